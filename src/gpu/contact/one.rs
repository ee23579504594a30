//! The contact stage in one workgroup on the device (`shaders/contact_one.wgsl`, and `prep_one` in
//! `shaders/contact_search.wgsl`): on CPU adapters with a small contact set, `prep` and `plan` in
//! one dispatch, and the narrow phase, the gather, the one-workgroup Lagrange solve, `finish` and
//! the reports in one more, where the per-item kernels take eight. The items' arithmetic and the
//! order of every sum are those of the per-item kernels: the same bits (tested). The search between
//! the two stays as it is. Its pipelines, the choice of the path, and its dispatches. CPU
//! reference: [`crate::contact::ContactSet::apply`].

use super::kernels::{module, pipeline, Layouts};
use super::search::SearchKernels;
use super::{colouring, narrow, report, solve, Dispatch};
use crate::gpu::reduce::TREE;
use crate::gpu::shader::Features;

/// WGSL source (compiled after [`super::narrow::SOURCE`], [`super::colouring::SOURCE`],
/// [`super::solve::SOURCE`], the sum tree
/// ([`TREE`]) and [`super::report::SOURCE`]).
pub const SOURCE: &str = include_str!("../../../shaders/contact_one.wgsl");

/// The one-workgroup stage's shader module: its label and stage files (after
/// contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = (
    "contact_one",
    &[
        narrow::SOURCE,
        colouring::SOURCE,
        solve::SOURCE,
        TREE,
        report::SOURCE,
        SOURCE,
    ],
);

/// Contact nodes up to which a CPU adapter runs the contact stage in one workgroup.
///
/// On lavapipe every dispatch that has work costs 40 to 90 us on two threads whatever its size
/// (its threads woken and waited for), and the per-item path has eight a step; in one workgroup
/// the stage runs on one thread instead of two. Measured on this project's 2-core machine
/// (BENCHMARKS.md, 2026-11-25, 52afce8; the two paths alternated in one process, median us a
/// step): the pile of disks with 2 400 contact nodes (10^4 elements) 1 271 per item against
/// 1 140 in one workgroup, 5 400 nodes 2 695 against 2 638, 9 600 nodes 3 566 against 3 765,
/// 24 576 nodes (10^5 elements) 10 812 against 11 086; the 10^5-element striker (2 064 nodes)
/// 8 554 against 7 736.
pub const ONE_NODES: usize = 1 << 12;

/// Whether the contact stage runs in one workgroup for `nodes` contact nodes on an adapter of
/// `device_type` (CPU adapters only: on a GPU a dispatch costs a few microseconds, and one
/// workgroup would leave the rest of the device idle).
pub fn one_path(nodes: usize, device_type: wgpu::DeviceType) -> bool {
    device_type == wgpu::DeviceType::Cpu && nodes <= ONE_NODES
}

/// The one-workgroup stage's pipelines: `prep_one` (of the search's module) and `contact_one`.
#[derive(Debug)]
pub struct OneKernels {
    prep_one: wgpu::ComputePipeline,
    contact_one: wgpu::ComputePipeline,
}

impl OneKernels {
    /// Compiles the one-workgroup kernels (`prep_one` from the module of `search`).
    pub(crate) fn new(
        device: &wgpu::Device,
        layouts: &Layouts,
        features: Features,
        search: &SearchKernels,
    ) -> Self {
        let m = module(device, MODULE, features);
        OneKernels {
            prep_one: pipeline(device, &search.module, &layouts.with_indirect, "prep_one"),
            contact_one: pipeline(device, &m, &layouts.main, "contact_one"),
        }
    }

    /// Records `prep_one`: the node preparation and the search plan in one workgroup.
    pub(crate) fn record_prep(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.prep_one, 1);
    }

    /// Records `contact_one`: the stage after the search in one workgroup.
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.contact_one, 1);
    }
}
