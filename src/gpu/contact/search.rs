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

/// Contact nodes and slots (the larger) up to which a GPU searches in one workgroup
/// ([`search_one_path`]). On an NVIDIA H200 (2026-11-28, c2f47a1, the device check's steps 5 and
/// 9) one workgroup took the search part of the 10^4 striker from 22.9 to 17.0 us a step, and
/// that of the 10^5 striker from 30.7 to 43.0 us. Their contact nodes are the boundaries of the
/// striker's n x n quads and the plate's 5n x n, about 16 n: 656 at n = 41 and 2 064 at
/// n = 129. One workgroup then costs about 4.9 us plus 0.018 us an item, and the per-item
/// kernels' time grows by about 0.006 us an item: the two meet near 1 100 items.
pub const SEARCH_ONE_ITEMS: usize = 1 << 10;

/// Contact nodes and slots (the larger) up to which a GPU switches its search into one workgroup
/// while searches are rare ([`search_switch`]). On an NVIDIA H200 (2026-11-28, 1350d3a) the
/// 10^4-element pile (100 disks, about 3 600 contact nodes), which searched about once in 500
/// steps, took 14.5 us a step in the per-item kernels' search part and 6.3 us in one workgroup
/// (`step dev` 95.9 against 88.2 us); the 10^5 pile (about 36 000) 16.8 against 18.2 us, one search
/// in one workgroup then costing about 6.7 ms.
pub const SEARCH_ONE_RARE_ITEMS: usize = 1 << 13;

/// The default [`super::SearchSwitch`]: searches counted over 512 steps, one workgroup below one
/// search in 64 steps. The striker searches about once in 7 steps, the pile once in 500; by the
/// H200 figures above, a search in one workgroup of 8 192 items costs about 1 ms more than per
/// item, and the per-item kernels' empty dispatches about 13 us a step more than one workgroup's:
/// break-even near one search in 80 steps.
pub const SEARCH_SWITCH: super::SearchSwitch = super::SearchSwitch {
    window: 512,
    searches: 8,
};

/// Whether (and how) the search of `nodes` contact nodes and `slots` slots on an adapter of
/// `device_type` switches between its two ways by the searches' rate, by default: on GPUs between
/// [`SEARCH_ONE_ITEMS`] (below it always one workgroup) and [`SEARCH_ONE_RARE_ITEMS`] (beyond it
/// always per item), with [`SEARCH_SWITCH`]; never on CPU adapters.
pub fn search_switch(
    nodes: usize,
    slots: usize,
    device_type: wgpu::DeviceType,
) -> Option<super::SearchSwitch> {
    let n = nodes.max(slots);
    (device_type != wgpu::DeviceType::Cpu && n > SEARCH_ONE_ITEMS && n <= SEARCH_ONE_RARE_ITEMS)
        .then_some(SEARCH_SWITCH)
}

/// The most contact nodes and slots (the larger) with which a CPU adapter may be asked to search
/// in one workgroup ([`super::ContactOptions::search_one`]; it does not by default). llvmpipe
/// (lavapipe) ends a shader invocation's loops after 65 535 iterations in all
/// (`LP_MAX_TGSI_LOOP_ITERATIONS`, "shared between every loop" of a shader, Mesa's gallivm), and
/// one workgroup of 8 lanes takes every item of every stage in turn: the pile of 196 disks (9 408
/// slots) lost candidates that way on 2026-11-28, silently. At this bound the test scenes search
/// in one workgroup with the per-item kernels' bits.
pub const SEARCH_ONE_CPU_MAX: usize = 1 << 10;

/// Whether the search runs in one workgroup (`search_one` in `shaders/contact_search.wgsl`) for
/// `nodes` contact nodes and `slots` slots on an adapter of `device_type`, rather than in its
/// eleven per-item kernels: on a GPU up to [`SEARCH_ONE_ITEMS`] of each, on a CPU adapter never
/// ([`SEARCH_ONE_CPU_MAX`]). The per-item kernels are dispatched on every step, empty (zero
/// workgroups) on the steps that do not search, and each costs its dispatch and the barrier
/// before it; one workgroup takes one dispatch a step, and more time on the steps that search,
/// in proportion to the items over its 256 threads.
pub fn search_one_path(nodes: usize, slots: usize, device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu && nodes.max(slots) <= SEARCH_ONE_ITEMS
}

impl super::ContactState {
    /// After a readback at step `step` (the counters just read): at the end of the search
    /// switch's window, the next steps search in one workgroup when the window had fewer than
    /// the switch's searches per its window of steps, else per item ([`super::SearchSwitch`]).
    /// Returns whether the way changed (the commands a step records change with it).
    pub(crate) fn switch_search(&mut self, step: u32) -> bool {
        let Some((s, from, searches)) = self.search_switch else {
            return false;
        };
        let steps = step.saturating_sub(from);
        if steps < s.window {
            return false;
        }
        let now = self.counters.searches;
        let one = u64::from(now.saturating_sub(searches)) * u64::from(s.window)
            < u64::from(s.searches) * u64::from(steps);
        self.search_switch = Some((s, step, now));
        if one == self.search_one {
            return false;
        }
        self.search_one = one;
        self.search_switches += 1;
        true
    }

    /// Times the search switched its way so far ([`super::SearchSwitch`]).
    pub fn search_switches(&self) -> u64 {
        self.search_switches
    }
}

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
    search_one: wgpu::ComputePipeline,
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
            search_one: pipeline(device, &m, &layouts.main, "search_one"),
            module: m,
        }
    }

    /// Records the node preparation and the search plan (`prep`, `plan`).
    pub(crate) fn record_prep(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.prep, groups(d.params.n_local));
        d.direct(pass, &self.plan, 1);
    }

    /// Records the search in one workgroup (`search_one`; [`search_one_path`]): one direct
    /// dispatch, empty when no search is due.
    pub(crate) fn record_one(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.search_one, 1);
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
