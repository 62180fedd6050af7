//! Choosing an adapter and opening a device, for the window and for offscreen capture.

use crate::AppError;

/// An open device and what it runs on.
pub struct Gpu {
    /// The instance the adapter came from (the window creates its surface from it).
    pub instance: wgpu::Instance,
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

/// Backends from `WGPU_BACKEND` if set, else all of them.
pub fn backends() -> wgpu::Backends {
    wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all())
}

/// Preference among adapters: a real GPU first, the software rasteriser (llvmpipe) last.
fn rank(info: &wgpu::AdapterInfo) -> u32 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// Opens the best adapter with no window: a real GPU if there is one, else the software
/// rasteriser (Mesa llvmpipe through the GL backend on a machine without a GPU).
/// `WGPU_ADAPTER_NAME` (a substring) picks one by name.
pub fn offscreen() -> Result<Gpu, AppError> {
    let backends = backends();
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends,
        ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
    });
    let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted = wanted.to_lowercase();
        adapters.retain(|a| a.get_info().name.to_lowercase().contains(&wanted));
    }
    adapters.sort_by_key(|a| rank(&a.get_info()));
    let adapter = adapters.into_iter().next().ok_or_else(|| {
        AppError::Gpu(format!(
            "no graphics adapter found (backends {backends:?}); install a GPU driver or Mesa's \
             llvmpipe (libegl1 + libgl1-mesa-dri), or set WGPU_BACKEND"
        ))
    })?;
    open(instance, adapter)
}

/// Opens a device on `adapter` with limits any adapter, llvmpipe on GL included, offers.
pub fn open(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Gpu, AppError> {
    let info = adapter.get_info();
    log::info!(
        "adapter: {} ({:?}, {:?})",
        info.name,
        info.backend,
        info.device_type
    );
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("ragdoll-lab"),
        required_features: wgpu::Features::empty(),
        required_limits:
            wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits()),
        ..Default::default()
    }))
    .map_err(|e| AppError::Gpu(format!("cannot open a device on {}: {e}", info.name)))?;
    Ok(Gpu {
        instance,
        adapter,
        device,
        queue,
    })
}

/// The MSAA sample count to use for `format`: 4 where the adapter supports it, else 1.
pub fn msaa_samples(adapter: &wgpu::Adapter, format: wgpu::TextureFormat) -> u32 {
    let flags = adapter.get_texture_format_features(format).flags;
    let depth = adapter
        .get_texture_format_features(super::DEPTH_FORMAT)
        .flags;
    if flags.sample_count_supported(4) && depth.sample_count_supported(4) {
        4
    } else {
        1
    }
}
