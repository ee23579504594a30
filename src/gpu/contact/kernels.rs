//! The compiled contact kernels ([`ContactKernels`]: each stage's, built by its file, stateless
//! and compiled once per device) and what they share: the shader modules' sources
//! ([`MODULES`], [`stage_source`]) and the layouts of the bind groups every contact kernel binds
//! (`Layouts`). The buffers they bind are the contact state's ([`super::ContactState`]).

use std::borrow::Cow;

use super::{narrow, one, report, search, solve, COMMON};
use crate::gpu::shader;
use crate::gpu::shader::Features;

/// The contact shader modules: each one's label and stage files (after contact_common.wgsl).
pub const MODULES: [(&str, &[&str]); 5] = [
    search::MODULE,
    narrow::MODULE,
    solve::MODULE,
    report::MODULE,
    one::MODULE,
];

/// The complete source of a contact stage: common.wgsl, contact_common.wgsl, then `parts`.
pub fn stage_source(parts: &[&str], features: Features) -> String {
    let mut kernel = String::from(COMMON);
    for p in parts {
        kernel.push('\n');
        kernel.push_str(p);
    }
    shader::source(&kernel, features)
}

/// Compiles the contact shader module `(label, parts)` (one of [`MODULES`]).
pub(crate) fn module(
    device: &wgpu::Device,
    (label, parts): (&str, &[&str]),
    features: Features,
) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(Cow::Owned(stage_source(parts, features))),
    })
}

/// The pipeline of entry point `entry` of `module` with `layout`.
pub(crate) fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A read-write storage buffer at `binding` (every contact binding but the index entry).
pub(super) fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform buffer at `binding`, with a dynamic offset when `dynamic`.
fn uniform_entry(binding: u32, dynamic: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Declares a contact stage's kernels: a struct with one pipeline per entry point of the stage's
/// module (the `MODULE` of the file that invokes it), each field named for its entry point, all
/// with group 0 alone ([`Layouts::main`]), and its `new`, which compiles them once per device.
macro_rules! stage_kernels {
    ($(#[$doc:meta])* $name:ident: $($entry:ident),+) => {
        $(#[$doc])*
        #[derive(Debug)]
        pub struct $name {
            $($entry: wgpu::ComputePipeline,)+
        }

        impl $name {
            /// Compiles the stage's module and its pipelines.
            pub(crate) fn new(
                device: &wgpu::Device,
                layouts: &$crate::gpu::contact::kernels::Layouts,
                features: $crate::gpu::shader::Features,
            ) -> Self {
                let m = $crate::gpu::contact::kernels::module(device, MODULE, features);
                $name {
                    $($entry: $crate::gpu::contact::kernels::pipeline(
                        device,
                        &m,
                        &layouts.main,
                        stringify!($entry),
                    ),)+
                }
            }
        }
    };
}

pub(crate) use stage_kernels;

/// The layouts of the contact kernels: group 0, the buffers every contact kernel binds
/// (`shaders/contact_common.wgsl`'s bindings 1 to 17, the index entry by dynamic offset), and
/// group 1 of the kernels that write indirect sizes ([`search::indirect_layout`]).
#[derive(Debug)]
pub(crate) struct Layouts {
    /// Group 0.
    pub shared: wgpu::BindGroupLayout,
    /// Group 1.
    pub indirect: wgpu::BindGroupLayout,
    /// Group 0 alone.
    pub main: wgpu::PipelineLayout,
    /// Groups 0 and 1.
    pub with_indirect: wgpu::PipelineLayout,
}

impl Layouts {
    fn new(device: &wgpu::Device) -> Self {
        let mut entries = Vec::new();
        entries.extend((1..=16).filter(|&b| b != 10).map(storage_entry));
        entries.push(uniform_entry(17, true));
        let shared = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("contact"),
            entries: &entries,
        });
        let indirect = search::indirect_layout(device);
        let main = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("contact"),
            bind_group_layouts: &[Some(&shared)],
            immediate_size: 0,
        });
        let with_indirect = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("contact_indirect"),
            bind_group_layouts: &[Some(&shared), Some(&indirect)],
            immediate_size: 0,
        });
        Layouts {
            shared,
            indirect,
            main,
            with_indirect,
        }
    }
}

/// The compiled contact kernels, by stage, and their layouts (stateless, built once per device).
#[derive(Debug)]
pub struct ContactKernels {
    pub(super) layouts: Layouts,
    pub(super) search: search::SearchKernels,
    pub(super) narrow: narrow::NarrowKernels,
    pub(super) solve: solve::SolveKernels,
    pub(super) report: report::ReportKernels,
    pub(super) one: one::OneKernels,
}

impl ContactKernels {
    /// Compiles the contact kernels.
    pub fn new(device: &wgpu::Device, features: Features) -> Self {
        let layouts = Layouts::new(device);
        let search = search::SearchKernels::new(device, &layouts, features);
        let narrow = narrow::NarrowKernels::new(device, &layouts, features);
        let solve = solve::SolveKernels::new(device, &layouts, features);
        let report = report::ReportKernels::new(device, &layouts, features);
        let one = one::OneKernels::new(device, &layouts, features, &search);
        ContactKernels {
            layouts,
            search,
            narrow,
            solve,
            report,
            one,
        }
    }
}
