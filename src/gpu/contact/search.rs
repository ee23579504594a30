//! Contact search on the device (`shaders/contact_search.wgsl`): positions of the step, whether a
//! search is due, the hashed uniform grid over the swept segment boxes, candidate lists per slot,
//! the node adjacency and the Jones-Plassmann colouring of the slots; its kernels' pipelines, the
//! group of the indirect sizes that `plan` and `scan_lists` write, and their dispatches. CPU
//! reference of the candidates: [`crate::contact`]'s parry broad phase (`crate::contact::broad`,
//! `crate::contact::search`; the GPU's candidates are a superset of the pairs it activates;
//! tested); of the colouring: [`coloring_is_proper`].

use super::kernels::{module, pipeline, Layouts};
use super::{groups, Dispatch};
use crate::gpu::shader::Features;

/// WGSL source.
pub const SOURCE: &str = include_str!("../../../shaders/contact_search.wgsl");

/// The search's shader module: its label and stage files (after contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = ("contact_search", &[SOURCE]);

/// Indirect-argument entries of the search kernels, in dispatch order (WGSL `plan`).
pub(crate) const ENTRIES: [&str; 14] = [
    "boxes",
    "seg_count",
    "scan_buckets",
    "seg_fill",
    "slot_count",
    "scan_slots",
    "slot_fill",
    "adj_count",
    "scan_nodes",
    "adj_fill",
    "adj_sort",
    "color_round",
    "list_count",
    "list_fill",
];

/// The first of [`ENTRIES`] that colour the slots (only the per-colour solve needs them): the
/// colouring rounds, one dispatch each.
const COLOR_ROUND: usize = 11;
/// The entry of [`ENTRIES`] before which `scan_lists` (a direct dispatch) runs.
const LIST_FILL: usize = 13;

const _: () = assert!(matches!(ENTRIES[COLOR_ROUND].as_bytes(), b"color_round"));
const _: () = assert!(matches!(ENTRIES[LIST_FILL].as_bytes(), b"list_fill"));

/// The layout of group 1 of the kernels that write indirect sizes (`plan`, `scan_lists`, and
/// `prep_one` of [`super::one`]): the indirect-argument buffer.
pub(crate) fn indirect_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("contact_indirect"),
        entries: &[super::kernels::storage_entry(0)],
    })
}

/// Group 1 ([`indirect_layout`]) on the contact state's indirect-argument buffer `ind` (built
/// once).
pub(crate) fn bind_indirect(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    ind: &wgpu::Buffer,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("contact_indirect"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: ind.as_entire_binding(),
        }],
    })
}

/// The search's pipelines, and its module (whose `prep_one` the one-workgroup stage compiles).
#[derive(Debug)]
pub struct SearchKernels {
    pub(super) module: wgpu::ShaderModule,
    prep: wgpu::ComputePipeline,
    plan: wgpu::ComputePipeline,
    /// The kernels dispatched indirectly, in [`ENTRIES`] order.
    kernels: Vec<wgpu::ComputePipeline>,
    scan_lists: wgpu::ComputePipeline,
}

impl SearchKernels {
    /// Compiles the search kernels.
    pub(crate) fn new(device: &wgpu::Device, layouts: &Layouts, features: Features) -> Self {
        let m = module(device, MODULE, features);
        SearchKernels {
            prep: pipeline(device, &m, &layouts.main, "prep"),
            plan: pipeline(device, &m, &layouts.with_indirect, "plan"),
            kernels: ENTRIES
                .iter()
                .map(|e| pipeline(device, &m, &layouts.main, e))
                .collect(),
            scan_lists: pipeline(device, &m, &layouts.with_indirect, "scan_lists"),
            module: m,
        }
    }

    /// Records the node preparation and the search plan (`prep`, `plan`).
    pub(crate) fn record_prep(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.prep, groups(d.params.n_local));
        d.direct(pass, &self.plan, 1);
    }

    /// Records the search kernels, dispatched indirectly (empty when no search is due): the
    /// colouring only for the per-colour solve (the one-workgroup solve colours the step's
    /// constraints itself), one dispatch per colouring round.
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        let p = d.params;
        for (e, pl) in self.kernels.iter().enumerate() {
            if p.multi == 0 && e >= COLOR_ROUND {
                break;
            }
            if e == COLOR_ROUND {
                pass.set_pipeline(pl);
                for r in 0..p.jp_rounds {
                    d.bind(pass, r as u64);
                    d.indirect(pass, e as u64);
                }
                d.bind(pass, 0);
                continue;
            }
            if e == LIST_FILL {
                d.direct(pass, &self.scan_lists, 1);
            }
            pass.set_pipeline(pl);
            d.indirect(pass, e as u64);
        }
    }
}

/// Whether `color` (one per slot) is a proper colouring of the slots whose touched nodes are
/// `touched` (a slot's slave and its candidates' nodes): no two slots of one colour share a node.
pub fn coloring_is_proper(touched: &[Vec<u32>], color: &[u32]) -> bool {
    let mut seen: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    for (k, set) in touched.iter().enumerate() {
        let mut nodes = set.clone();
        nodes.sort_unstable();
        nodes.dedup();
        for n in nodes {
            if let Some(&other) = seen.get(&(n, color[k])) {
                if other != k {
                    return false;
                }
            }
            seen.insert((n, color[k]), k);
        }
    }
    true
}
