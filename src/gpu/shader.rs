//! WGSL sources: each kernel's file with `shaders/common.wgsl` prepended, and `//#if NAME` ...
//! `//#else` / `//#endif` blocks kept only for the features a scene needs (so a scene without, say, velocity
//! boundaries compiles no binding for them); `compute_pipeline` compiles one into a pipeline.

use std::borrow::Cow;

use crate::error::{Error, Result};

/// Shared declarations prepended to every kernel.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");

/// Optional parts of the kernels, and the reduction workgroup size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Features {
    /// Dissipative element state (viscous hourglass or bulk viscosity).
    pub dissipation: bool,
    /// Field snapshots.
    pub fields: bool,
    /// Pressure loads, mass damping or gravity: the node stage keeps v^{n-1/2} for their work
    /// (and damps, and adds m g).
    pub loads: bool,
    /// J2 plastic bodies: the element stage keeps a plastic state per element.
    pub plastic: bool,
    /// Axisymmetric bodies: the element stage's hoop terms, and the dissipative element state
    /// keeps the hoop bulk stress.
    pub axisymmetric: bool,
    /// Linear elastic bodies: the element stage's small-strain branch.
    pub linear_elastic: bool,
    /// Neo-Hookean bodies: the element stage's hyperelastic branch.
    pub neo_hookean: bool,
    /// Plane stress bodies: the neo-Hookean branch's Newton iteration for the out-of-plane
    /// stretch.
    pub plane_stress: bool,
    /// Bodies with the stiffness hourglass form.
    pub hourglass_stiffness: bool,
    /// Materials with `failure`: the element stage's failure check and erosion state (a scene
    /// without failure compiles neither, nor their bindings).
    pub failure: bool,
    /// Materials with Johnson-Cook thermal softening: the element stage's temperature (in the
    /// plastic state, no buffer of its own), softening and heating, and the damage's d5 term (a
    /// scene without compiles none of it).
    pub thermal: bool,
    /// Contacts or walls by penalty, perturbed or augmented Lagrangian (WGSL `SPRINGS`).
    pub contact_springs: bool,
    /// Contacts or walls with Coulomb friction (WGSL `FRICTION`).
    pub contact_friction: bool,
    /// Threads per workgroup of the reductions and control kernels (WGSL `RG`): 256 on GPUs,
    /// 64 on CPU adapters such as lavapipe, where each barrier costs a coroutine switch per lane group.
    pub reduce_group: u32,
    /// Threads of the run control kernels' one workgroup (WGSL `RG` of `shaders/control.wgsl`):
    /// 256 on GPUs, 8 on CPU adapters, where every barrier of its trees switches each lane
    /// group's coroutine ([`crate::gpu::control`]).
    pub control_group: u32,
    /// Threads of the one-workgroup contact kernels (WGSL `SG`: the search's scans, the
    /// one-workgroup Lagrange solve, the reports' end): 256 on GPUs, 8 on CPU adapters
    /// ([`crate::gpu::contact::one_group`]).
    pub contact_group: u32,
    /// Lagrange constraints the one-workgroup solve compacts and colours in workgroup memory
    /// (WGSL `CAP`; more take the slower path through storage, with the same result), from the
    /// device's workgroup storage ([`local_constraints`]).
    pub contact_cap: u32,
    /// Whether the one-workgroup solve colours its constraints in parallel rounds in a hashed
    /// order (WGSL `PARALLEL_COLOURING`; [`crate::gpu::contact::colouring`]) or greedily in slot
    /// order in one invocation (CPU adapters: [`crate::gpu::contact::parallel_colouring`]).
    pub contact_parallel_colouring: bool,
    /// Whether the one-workgroup solve pairs the two constraints of a node pair met from both
    /// passes and solves them as a 2 x 2 block (WGSL `PAIR_BLOCKS`; GPUs:
    /// [`crate::gpu::contact::pair_blocks`]): compiled out otherwise.
    pub contact_pair_blocks: bool,
    /// Whether the one-workgroup solve's sweeps keep the packed nodes' records and the
    /// multipliers in workgroup memory where they fit (WGSL `LOCAL_SWEEPS`; GPUs:
    /// [`crate::gpu::contact::local_sweeps`]), or read and write them through storage (CPU
    /// adapters): the same bits either way.
    pub contact_local_sweeps: bool,
}

/// Threads per workgroup of the per-item contact kernels (`crate::gpu::contact::CG`).
pub const ITEM_GROUP: u32 = 64;

/// Lagrange constraints the one-workgroup solve compacts and colours in workgroup memory (WGSL
/// `CAP`, 28 bytes each, with at most 1.5 `CAP` distinct nodes) on a device with `storage` bytes
/// of workgroup storage and the one-workgroup kernels at `group` threads: what the other
/// workgroup arrays of the contact kernels leave (at most 40 bytes per thread of `group`, 16 per
/// thread of the per-item kernels, and 1 KiB), in multiples of 32, from 32 to 2048 (the ranks of
/// `contact_colour.wgsl` hold a constraint's index in 12 bits). A step with more takes the
/// compaction through storage, with the same colours: its rounds read each constraint's
/// neighbours from the search's node adjacency in storage, where the workgroup's read keys in its
/// own memory.
pub fn local_constraints(storage: u32, group: u32) -> u32 {
    let others = 40 * group + 16 * ITEM_GROUP + 1024;
    (storage.saturating_sub(others) / 28 / 32 * 32).clamp(32, 2048)
}

impl Default for Features {
    fn default() -> Self {
        Self {
            dissipation: false,
            fields: false,
            loads: false,
            plastic: false,
            axisymmetric: false,
            linear_elastic: true,
            neo_hookean: true,
            plane_stress: true,
            hourglass_stiffness: true,
            failure: false,
            thermal: false,
            contact_springs: true,
            contact_friction: true,
            reduce_group: 256,
            control_group: 256,
            contact_group: 256,
            contact_cap: local_constraints(
                wgpu::Limits::default().max_compute_workgroup_storage_size,
                256,
            ),
            contact_parallel_colouring: true,
            contact_pair_blocks: true,
            contact_local_sweeps: true,
        }
    }
}

impl Features {
    fn enabled(&self, name: &str) -> bool {
        match name {
            "dissipation" => self.dissipation,
            "fields" => self.fields,
            "loads" => self.loads,
            "plastic" => self.plastic,
            "axisymmetric" => self.axisymmetric,
            "linear_elastic" => self.linear_elastic,
            "neo_hookean" => self.neo_hookean,
            "plane_stress" => self.plane_stress,
            "hourglass_stiffness" => self.hourglass_stiffness,
            "failure" => self.failure,
            "thermal" => self.thermal,
            _ => false,
        }
    }

    /// Every combination, for validation tests.
    pub fn all() -> Vec<Features> {
        let mut v = Vec::new();
        for dissipation in [false, true] {
            for fields in [false, true] {
                for loads in [false, true] {
                    for (plastic, axisymmetric, failure, thermal) in [
                        (false, false, false, false),
                        (true, true, true, true),
                        (true, false, true, false),
                        (true, false, false, true),
                    ] {
                        for (reduce_group, control_group, contact_group) in
                            [(64, 8, 8), (256, 256, 256)]
                        {
                            for elastic in [false, true] {
                                v.push(Features {
                                    dissipation,
                                    fields,
                                    loads,
                                    plastic,
                                    axisymmetric,
                                    linear_elastic: elastic,
                                    neo_hookean: elastic,
                                    plane_stress: elastic,
                                    hourglass_stiffness: elastic,
                                    failure,
                                    thermal,
                                    contact_springs: elastic,
                                    contact_friction: elastic,
                                    reduce_group,
                                    control_group,
                                    contact_group,
                                    contact_cap: local_constraints(
                                        wgpu::Limits::default().max_compute_workgroup_storage_size,
                                        contact_group,
                                    ),
                                    contact_parallel_colouring: contact_group > 8,
                                    contact_pair_blocks: !elastic,
                                    contact_local_sweeps: contact_group > 8,
                                });
                            }
                        }
                    }
                }
            }
        }
        v
    }
}

/// The complete source of a kernel for `features`.
pub fn source(kernel: &str, features: Features) -> String {
    let mut out = String::with_capacity(COMMON.len() + kernel.len());
    out.push_str(COMMON);
    out.push('\n');
    let mut keep = vec![true];
    'lines: for line in kernel.lines() {
        let t = line.trim();
        if let Some(name) = t.strip_prefix("//#if ") {
            let outer = *keep.last().unwrap_or(&true);
            keep.push(outer && features.enabled(name.trim()));
            continue;
        }
        if t == "//#else" {
            if keep.len() > 1 {
                let inner = keep.pop().unwrap_or(true);
                let outer = *keep.last().unwrap_or(&true);
                keep.push(outer && !inner);
            }
            continue;
        }
        if t == "//#endif" {
            if keep.len() > 1 {
                keep.pop();
            }
            continue;
        }
        if *keep.last().unwrap_or(&true) {
            if t == "const RG: u32 = 256u;" {
                out.push_str(&format!("const RG: u32 = {}u;\n", features.reduce_group));
                continue;
            }
            if t == "const CAP: u32 = 1024u;" {
                out.push_str(&format!("const CAP: u32 = {}u;\n", features.contact_cap));
                continue;
            }
            if t.starts_with("const CAP_SIZE: u32 = 1024u;") {
                let size = features.contact_cap.max(1);
                out.push_str(&format!("const CAP_SIZE: u32 = {size}u;\n"));
                continue;
            }
            if t == "const SG: u32 = 256u;" {
                out.push_str(&format!("const SG: u32 = {}u;\n", features.contact_group));
                continue;
            }
            for (name, on) in [
                ("SPRINGS", features.contact_springs),
                ("FRICTION", features.contact_friction),
                ("PARALLEL_COLOURING", features.contact_parallel_colouring),
                ("PAIR_BLOCKS", features.contact_pair_blocks),
                ("LOCAL_SWEEPS", features.contact_local_sweeps),
            ] {
                if t.starts_with(&format!("const {name}: bool = true;")) {
                    out.push_str(&line.replacen("true", if on { "true" } else { "false" }, 1));
                    out.push('\n');
                    continue 'lines;
                }
            }
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The compute pipeline of entry point `entry` of kernel source `kernel` (labelled `label`) with
/// the features `features` compiled in and, when given, the workgroup size `WG`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    kernel: &str,
    features: Features,
    entry: &str,
    workgroup: Option<u32>,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(Cow::Owned(source(kernel, features))),
    });
    let constants: Vec<(&str, f64)> = workgroup
        .map(|w| vec![("WG", w as f64)])
        .unwrap_or_default();
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// Parses and validates WGSL with naga (no GPU needed).
///
/// # Errors
/// [`Error::Gpu`] with naga's message.
pub fn validate(name: &str, wgsl: &str) -> Result<()> {
    let module = naga::front::wgsl::parse_str(wgsl)
        .map_err(|e| Error::Gpu(format!("{name}: {}", e.emit_to_string(wgsl))))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| Error::Gpu(format!("{name}: {e:?}")))?;
    Ok(())
}
