//! The headless GPU context: instance from the environment, the adapter [`super::choice`] picks
//! (by index, PCI bus id or name, within `CUDA_VISIBLE_DEVICES` / `ROCR_VISIBLE_DEVICES`),
//! device and queue, and the kernels compiled on it ([`KernelCache`]: one compilation per
//! combination of features for the context's life).

use std::sync::{Arc, Mutex, OnceLock};

use super::choice::{arrange, choose, Candidate, Selector, Visible};
use super::kernels::{Features, Kernels};
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
    /// The kernels compiled on `device` so far.
    pub kernels: KernelCache,
}

/// The kernels compiled on one device, by what they were compiled for: a second solver with the
/// same features (the cases of a verification ladder, a bench's sizes, a study or the tests in
/// one process) reuses the pipelines instead of compiling them again. Compiling the contact
/// kernels costs lavapipe about 2.5 s of CPU with Mesa's shader cache warm and about 28 s cold
/// (measured 2026-11-27 on a 2-core AMD EPYC, Mesa 22.3.6): half of the GPU tests' CPU time was
/// spent there. Pipelines are immutable and hold no simulation state, so sharing them changes
/// no result. At most [`KernelCache::CAPACITY`] entries; the oldest leaves first.
#[derive(Debug, Default)]
pub struct KernelCache {
    entries: Mutex<Vec<(KernelKey, Arc<Kernels>)>>,
}

/// What a set of kernels was compiled for: the features and the optional stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct KernelKey {
    /// Features compiled in.
    pub features: Features,
    /// Velocity boundaries.
    pub boundaries: bool,
    /// Contact or rigid walls.
    pub contact: bool,
    /// Pressure loads.
    pub pressure: bool,
}

impl KernelCache {
    /// Most sets of kernels kept.
    pub const CAPACITY: usize = 32;

    /// The kernels for `key`, compiled by `compile` unless a set was kept; `compile` returns
    /// `None` when the device rejected them, and nothing is kept then.
    pub fn get_or_compile(
        &self,
        key: KernelKey,
        compile: impl FnOnce() -> Option<Kernels>,
    ) -> Option<Arc<Kernels>> {
        if let Some(k) = self.find(&key) {
            return Some(k);
        }
        // Compiled outside the lock: two threads asking for the same new key may both compile
        // it (the same pipelines); the first kept is used from then on.
        let compiled = Arc::new(compile()?);
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, k)) = entries.iter().find(|(k, _)| *k == key) {
            return Some(k.clone());
        }
        if entries.len() >= Self::CAPACITY {
            entries.remove(0);
        }
        entries.push((key, compiled.clone()));
        Some(compiled)
    }

    fn find(&self, key: &KernelKey) -> Option<Arc<Kernels>> {
        let entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        entries
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, k)| k.clone())
    }

    /// Sets of kernels kept.
    pub fn len(&self) -> usize {
        self.entries.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// Whether none is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
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

/// The adapters a run may open, in the order `--adapter INDEX` counts them
/// ([`super::choice::arrange`]: by kind, then PCI bus id; within `CUDA_VISIBLE_DEVICES` and
/// `ROCR_VISIBLE_DEVICES`), as `(description, is software)`.
///
/// # Errors
/// [`Error::Gpu`] for a visibility variable that cannot be mapped (a UUID).
pub fn visible_adapters() -> Result<Vec<(String, bool)>> {
    let inst = instance();
    let adapters = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
    let infos: Vec<wgpu::AdapterInfo> = adapters.iter().map(|a| a.get_info()).collect();
    let candidates: Vec<Candidate> = infos.iter().map(Candidate::from).collect();
    let order = arrange(&candidates, &Visible::from_env()).map_err(Error::Gpu)?;
    Ok(order
        .into_iter()
        .map(|i| {
            (
                describe(&infos[i]),
                infos[i].device_type == wgpu::DeviceType::Cpu,
            )
        })
        .collect())
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
    /// Opens the adapter that `adapter` names ([`Selector::parse`]: an index into the list of
    /// [`visible_adapters`], a PCI bus id, or a substring of the name, case-insensitive), or else
    /// the one whose name contains `WGPU_ADAPTER_NAME`, or else the first of the list (the most
    /// capable kind: discrete, integrated, virtual, CPU), among the adapters that
    /// `CUDA_VISIBLE_DEVICES` and `ROCR_VISIBLE_DEVICES` leave ([`super::choice`]).
    ///
    /// # Errors
    /// [`Error::Gpu`] naming the adapters found when none exists or none matches, or for a
    /// visibility variable that cannot be mapped.
    pub fn new(adapter: Option<&str>) -> Result<GpuContext> {
        let inst = instance();
        let adapters = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
        let selector = match adapter.filter(|s| !s.trim().is_empty()) {
            Some(a) => Some(Selector::parse(a)),
            None => std::env::var("WGPU_ADAPTER_NAME")
                .ok()
                .filter(|s| !s.is_empty())
                .map(Selector::Name),
        };
        let candidates: Vec<Candidate> = adapters
            .iter()
            .map(|a| Candidate::from(&a.get_info()))
            .collect();
        let chosen =
            choose(&candidates, selector.as_ref(), &Visible::from_env()).map_err(Error::Gpu)?;
        let Some(adapter) = adapters.into_iter().nth(chosen) else {
            return Err(Error::Gpu(format!("adapter {chosen} vanished")));
        };
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut limits = wgpu::Limits::default();
        let al = adapter.limits();
        limits.max_storage_buffers_per_shader_stage =
            al.max_storage_buffers_per_shader_stage.min(16);
        limits.max_storage_buffer_binding_size = al.max_storage_buffer_binding_size;
        limits.max_buffer_size = al.max_buffer_size;
        limits.max_compute_workgroups_per_dimension = al.max_compute_workgroups_per_dimension;
        // The one-workgroup contact solve keeps as much of its work in workgroup memory as fits
        // (crate::gpu::shader::local_constraints).
        limits.max_compute_workgroup_storage_size = al.max_compute_workgroup_storage_size;
        // And up to 1024 threads in a workgroup where the adapter has them
        // (`ContactOptions::group`; the default groups stay within wgpu's default 256).
        limits.max_compute_invocations_per_workgroup =
            al.max_compute_invocations_per_workgroup.min(1024);
        limits.max_compute_workgroup_size_x = al.max_compute_workgroup_size_x.min(1024);
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
            kernels: KernelCache::default(),
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
