//! The headless GPU context: instance from the environment, adapter by name, device and queue.

use std::sync::{Arc, OnceLock};

use crate::error::{Error, Result};

/// A device and queue on a chosen adapter.
#[derive(Debug)]
pub struct GpuContext {
    /// Device.
    pub device: wgpu::Device,
    /// Queue.
    pub queue: wgpu::Queue,
    /// What the adapter says of itself.
    pub info: wgpu::AdapterInfo,
    /// Whether timestamp queries are available (used only when present).
    pub timestamps: bool,
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    // Indirect dispatch sizes are written by our own control kernel and bounded by construction;
    // skip wgpu's validation pass for them (it doubles the dispatches of a step).
    desc.flags = wgpu::InstanceFlags::empty();
    let desc = desc.with_env();
    let mut desc = desc;
    if std::env::var_os("WGPU_BACKEND").is_none() {
        // Compute only: Vulkan, Metal and DX12 (GL lacks what the kernels need on some drivers).
        desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12;
    }
    wgpu::Instance::new(desc)
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

/// Names of the adapters the environment offers.
pub fn adapters() -> Vec<String> {
    let inst = instance();
    pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| describe(&a.get_info()))
        .collect()
}

impl GpuContext {
    /// Opens the adapter whose name contains `name` (case-insensitive), or else the one named by
    /// `WGPU_ADAPTER_NAME`, or else the most capable one (discrete, integrated, virtual, CPU).
    ///
    /// # Errors
    /// [`Error::Gpu`] naming the adapters found when none exists or none matches.
    pub fn new(name: Option<&str>) -> Result<GpuContext> {
        let inst = instance();
        let adapters = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
        let wanted = name
            .map(str::to_string)
            .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
            .filter(|s| !s.is_empty());
        let found: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
        let rank = |t: wgpu::DeviceType| match t {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        let adapter = adapters
            .into_iter()
            .filter(|a| match &wanted {
                Some(w) => a.get_info().name.to_lowercase().contains(&w.to_lowercase()),
                None => true,
            })
            .min_by_key(|a| rank(a.get_info().device_type))
            .ok_or_else(|| {
                Error::Gpu(match &wanted {
                    Some(w) => format!("no GPU adapter matches {w:?}; found: {found:?}"),
                    None => "no GPU adapter found (install a Vulkan driver, e.g. Mesa lavapipe: \
                             apt-get install mesa-vulkan-drivers)"
                        .to_string(),
                })
            })?;
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut limits = wgpu::Limits::default();
        let al = adapter.limits();
        limits.max_storage_buffers_per_shader_stage =
            al.max_storage_buffers_per_shader_stage.min(16);
        limits.max_storage_buffer_binding_size = al.max_storage_buffer_binding_size;
        limits.max_buffer_size = al.max_buffer_size;
        limits.max_compute_workgroups_per_dimension = al.max_compute_workgroups_per_dimension;
        let features = if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("ricochet"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("cannot open {}: {e}", describe(&info))))?;
        Ok(GpuContext {
            device,
            queue,
            info,
            timestamps,
        })
    }

    /// A process-wide context on the default adapter, opened once (for tests and benches).
    ///
    /// # Errors
    /// As [`GpuContext::new`], repeated on every call.
    pub fn shared() -> Result<Arc<GpuContext>> {
        static SHARED: OnceLock<std::result::Result<Arc<GpuContext>, String>> = OnceLock::new();
        SHARED
            .get_or_init(|| {
                GpuContext::new(None)
                    .map(Arc::new)
                    .map_err(|e| e.to_string())
            })
            .clone()
            .map_err(Error::Gpu)
    }

    /// Whether the adapter is a software implementation on the CPU (Mesa lavapipe / llvmpipe,
    /// WARP, SwiftShader): `--backend auto` prefers the CPU reference over it.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Adapter description for reports.
    pub fn adapter_name(&self) -> String {
        describe(&self.info)
    }
}
