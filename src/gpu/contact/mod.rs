//! Contact on the device, compiled, allocated and dispatched only for scenes with contact or
//! rigid walls. The step's CONTACT stage, by file (each beside its WGSL kernel):
//!
//! - [`search`]: positions of the step, whether a search is due, candidates from a hashed uniform
//!   grid, the active slots (those that can touch before the next search: a pass slot with
//!   candidates, a wall slot within the margin of its wall) and a colouring of the slots, all on
//!   the device (no readback of the nodes);
//! - [`narrow`]: each active slot's constraint, the penalty impulses and the Lagrange warm starts;
//! - [`solve`]: the diagonal-mass Lagrange correction (projected Gauss-Seidel by colours, in one
//!   workgroup or one dispatch per colour) and the active-set update;
//! - [`report`]: corrected velocities, u_{n+1}, the impulses' work and the interface reports;
//! - [`one`]: on CPU adapters with a small contact set, the stage in two one-workgroup dispatches
//!   (before and after the search) instead of eight.
//!
//! Every kernel binds the one bind group built here (one explicit layout). The host reads back
//! only the contact counters with each batch's control block; a search that needs more candidate
//! room or more colouring rounds stops the step before it changed anything, and
//! [`ContactState::grow`] enlarges what is needed and resumes the step. CPU reference:
//! [`crate::contact::ContactSet::apply`].
#![allow(missing_docs)]

pub mod narrow;
pub mod one;
pub mod report;
pub mod search;
pub mod solve;

use std::borrow::Cow;

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::model::Model;

use super::alloc::Alloc;
use super::shader;
use super::shader::Features;

/// Shared WGSL declarations of the contact kernels.
pub const COMMON: &str = include_str!("../../../shaders/contact_common.wgsl");

/// Control state set when a contact buffer must grow (WGSL `STATE_SEARCH_GROW`).
pub const STATE_SEARCH_GROW: u32 = 4;

/// [`ContactState::record_parts`]: the node preparation and the search plan.
pub const PART_PREP: u32 = 1;
/// [`ContactState::record_parts`]: the search kernels (empty dispatches when none is due).
pub const PART_SEARCH: u32 = 2;
/// [`ContactState::record_parts`]: the narrow phase and the gather of the constraints.
pub const PART_NARROW: u32 = 4;
/// [`ContactState::record_parts`]: the Lagrange correction (or the penalty forces).
pub const PART_SOLVE: u32 = 8;
/// [`ContactState::record_parts`]: the finish (node update) and the interface reports.
pub const PART_REPORT: u32 = 16;
/// [`ContactState::record_parts`]: the whole contact stage.
pub const PART_ALL: u32 = 31;
/// Colours at most (WGSL `MAX_COLORS`).
pub const MAX_COLORS: u32 = 64;
/// Sweep slots of the per-colour path (WGSL `MAX_SWEEP_SLOTS`).
pub const MAX_SWEEP_SLOTS: u32 = 80;
/// Threads per workgroup of the per-item kernels (WGSL `CG`).
pub const CG: u32 = 64;
/// Colouring rounds recorded at first.
pub const FIRST_ROUNDS: u32 = 24;
/// Indirect entry of the kernels over the active slots (narrow phase, slot reports; WGSL
/// `ACTIVE_ENTRY`), written at each search after the search kernels' and the colours' entries.
pub const ACTIVE_ENTRY: u32 = 14 + MAX_COLORS;
/// Stride of the dynamic-offset index entries.
const INDEX_STRIDE: u64 = 256;
/// Index entries: colouring rounds and re-checks first, then (colour, sweep) pairs.
const ROUND_ENTRIES: u64 = MAX_COLORS as u64;

const GROW_CANDIDATES: u32 = 1;
const GROW_COLORS: u32 = 2;
const GROW_ROUNDS: u32 = 4;

/// Mirror of WGSL `ContactParams`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct ContactParams {
    pub n_local: u32,
    pub n_slots: u32,
    pub n_segs: u32,
    pub n_ifaces: u32,
    pub margin: f32,
    pub max_sweeps: u32,
    pub multi: u32,
    pub hist_stride: u32,
    pub row_capacity: u32,
    pub n_buckets: u32,
    pub cand_capacity: u32,
    pub adj_capacity: u32,
    pub jp_rounds: u32,
    pub colors_recorded: u32,
    pub tolerance: f32,
    pub friction: u32,
    pub o_bcount: u32,
    pub o_boff: u32,
    pub o_bcur: u32,
    pub o_bent: u32,
    pub o_ccount: u32,
    pub o_coff: u32,
    pub o_ncount: u32,
    pub o_noff: u32,
    pub o_ncur: u32,
    pub o_color: u32,
    pub o_lcount: u32,
    pub o_loff: u32,
    pub o_lcur: u32,
    pub o_list: u32,
    pub o_iface: u32,
    pub o_act: u32,
    pub o_mask: u32,
    pub f_rf: u32,
    /// 1.0, read at run time (the report's compensated work sums; see `Params::one`).
    pub one: f32,
    /// Nodes of the model: `v_prev`'s second third (from this index) holds node.wgsl's velocity
    /// residuals, its last third (from twice this index) the displacement residuals, which the
    /// contact's corrections join.
    pub n_nodes: u32,
    pub f_box: u32,
    pub f_usearch: u32,
    pub f_rp: u32,
    pub f_wp: u32,
    /// ws offsets of the active slots (those that can have a constraint until the next search:
    /// a pass slot with candidates, a wall slot near its wall): a flag per slot, their
    /// exclusive prefix (n_slots + 1 words; the last is the count) and the list in slot order.
    pub o_aflag: u32,
    pub o_aoff: u32,
    pub o_alist: u32,
    /// 1: the one-workgroup solve's active-set re-checks run as their own dispatches over the
    /// active slots (`recheck_active`, many workgroups), between rounds of `solve_one`.
    pub split: u32,
    /// ws offsets of the one-workgroup solve's extrapolation (see
    /// [`crate::contact::extrapolation`]): (lambda, lt) after the last sweep per compacted
    /// constraint (2 words each), the nodes of the constraints, and their dv after the last sweep
    /// (2 words each).
    pub o_lprev: u32,
    pub o_nlist: u32,
    pub o_dvp: u32,
    /// 1: the one-workgroup solve extrapolates between sweeps (0: plain projected Gauss-Seidel;
    /// the per-colour path never does).
    pub extrapolate: u32,
    /// The one-workgroup solve's packed rows (`contact_solve.wgsl`, `pack`): ws offset of the
    /// compacted constraints' node indices into the packed nodes (3 words each), fws offsets of
    /// their rows (2 vec4 each), of their friction rows (1 vec4 each, with friction) and of the
    /// packed nodes (`n_local` + 1 vec4: dv and 1/m, the last one zero for walls).
    pub o_cidx: u32,
    pub f_row: u32,
    pub f_frow: u32,
    pub f_node: u32,
}

/// Mirror of the first part of WGSL `ContactCtl` (the counters the host reads back).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct ContactCounters {
    pub due: u32,
    pub extent: u32,
    pub n_cand: u32,
    pub need_cand: u32,
    pub n_adj: u32,
    pub searching: u32,
    pub n_colors: u32,
    pub searches: u32,
    pub grow: u32,
    pub lagrange: u32,
    /// Penalty impulses bounded so far (constraint-steps).
    pub bounded: u32,
    pub sweeps: u32,
    pub sweeps_total: u32,
    pub sweeps_max: u32,
    pub solve_steps: u32,
    pub unconverged: u32,
}

/// Bytes of WGSL `ContactParams`, at the start of `ContactCtl`.
pub const PARAMS_SIZE: u64 = std::mem::size_of::<ContactParams>() as u64;
/// Bytes of WGSL `ContactCtl`: the parameters, the counters, the per-sweep changes.
pub const CTL_SIZE: u64 = PARAMS_SIZE + 64 + 4 * MAX_SWEEP_SLOTS as u64 + 16;

/// Mirror of WGSL `Slot`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSlot {
    pub info: u32,
    pub s: u32,
    pub np: u32,
    pub nn: u32,
    pub normal: [f32; 2],
    pub point: [f32; 2],
    pub k: f32,
    pub pass: u32,
    pub body: u32,
    pub mu: f32,
    /// Penalty friction: the tangential spring over the normal one.
    pub kt: f32,
    /// Perturbed Lagrangian: the slots of the neighbours `np`, `nn` in the same pass (`NONE`:
    /// none), whose candidate segments give their gaps.
    pub ps: u32,
    pub ns: u32,
    /// Augmented Lagrangian: the multipliers' update rate (1/s; 0: another method).
    pub ar: f32,
}

/// Mirror of WGSL `Segment`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSegment {
    pub a: u32,
    pub b: u32,
    pub k: f32,
    pub pass: u32,
    pub body: u32,
    pub _pad: [u32; 3],
}

/// Size of WGSL `Cons` (scratch only).
pub const CONS_SIZE: u64 = 64;

const _: () = assert!(std::mem::size_of::<ContactParams>() == 208);
const _: () = assert!(std::mem::size_of::<ContactCounters>() == 64);
const _: () = assert!(std::mem::size_of::<GpuSlot>() == 64);
const _: () = assert!(std::mem::size_of::<GpuSegment>() == 32);

/// The compiled contact kernels and their layouts (stateless, built once per device).
#[derive(Debug)]
pub struct ContactKernels {
    layout: wgpu::BindGroupLayout,
    ind_layout: wgpu::BindGroupLayout,
    prep: wgpu::ComputePipeline,
    plan: wgpu::ComputePipeline,
    /// The search kernels dispatched indirectly, in [`search::ENTRIES`] order.
    search: Vec<wgpu::ComputePipeline>,
    scan_lists: wgpu::ComputePipeline,
    narrow: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    solve_one: wgpu::ComputePipeline,
    sweep_color: wgpu::ComputePipeline,
    recheck: wgpu::ComputePipeline,
    recheck_active: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    report_slots: wgpu::ComputePipeline,
    report_end: wgpu::ComputePipeline,
    prep_one: wgpu::ComputePipeline,
    contact_one: wgpu::ComputePipeline,
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
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

/// The contact shader modules: each one's label and stage files (after contact_common.wgsl).
pub const MODULES: [(&str, &[&str]); 5] = [
    ("contact_search", &[search::SOURCE]),
    ("contact_narrow", &[narrow::SOURCE]),
    ("contact_solve", &[narrow::SOURCE, solve::SOURCE]),
    ("contact_report", &[narrow::SOURCE, report::SOURCE]),
    (
        "contact_one",
        &[narrow::SOURCE, solve::SOURCE, report::SOURCE, one::SOURCE],
    ),
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

impl ContactKernels {
    /// Compiles the contact kernels.
    pub fn new(device: &wgpu::Device, features: Features) -> Self {
        let mut entries = Vec::new();
        entries.extend((1..=16).filter(|&b| b != 10).map(storage_entry));
        entries.push(uniform_entry(17, true));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("contact"),
            entries: &entries,
        });
        let ind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("contact_indirect"),
            entries: &[storage_entry(0)],
        });
        let main = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("contact"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let with_ind = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("contact_indirect"),
            bind_group_layouts: &[Some(&layout), Some(&ind_layout)],
            immediate_size: 0,
        });
        let module = |label: &str, parts: &[&str]| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(Cow::Owned(stage_source(parts, features))),
            })
        };
        let [search_m, narrow_m, solve_m, report_m, one_m] =
            MODULES.map(|(label, parts)| module(label, parts));
        let pipe = |m: &wgpu::ShaderModule, layout: &wgpu::PipelineLayout, entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(layout),
                module: m,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        ContactKernels {
            prep: pipe(&search_m, &main, "prep"),
            plan: pipe(&search_m, &with_ind, "plan"),
            search: search::ENTRIES
                .iter()
                .map(|e| pipe(&search_m, &main, e))
                .collect(),
            scan_lists: pipe(&search_m, &with_ind, "scan_lists"),
            narrow: pipe(&narrow_m, &main, "narrow"),
            gather: pipe(&narrow_m, &main, "gather"),
            solve_one: pipe(&solve_m, &main, "solve_one"),
            sweep_color: pipe(&solve_m, &main, "sweep_color"),
            recheck: pipe(&solve_m, &main, "recheck"),
            recheck_active: pipe(&solve_m, &main, "recheck_active"),
            finish: pipe(&report_m, &main, "finish"),
            report_slots: pipe(&report_m, &main, "report_slots"),
            report_end: pipe(&report_m, &main, "report_end"),
            prep_one: pipe(&search_m, &with_ind, "prep_one"),
            contact_one: pipe(&one_m, &main, "contact_one"),
            layout,
            ind_layout,
        }
    }
}

/// The shared buffers the contact kernels bind.
pub(crate) struct Shared<'a> {
    pub ctrl: &'a wgpu::Buffer,
    pub nodes: &'a wgpu::Buffer,
    pub v_prev: &'a wgpu::Buffer,
    pub sample_src: &'a wgpu::Buffer,
}

/// Offsets of the workspace arrays.
struct Workspace {
    words: u32,
    vec4s: u32,
}

fn layout_workspace(p: &mut ContactParams) -> Workspace {
    let mut at = 0u32;
    let mut take = |n: u32| {
        let o = at;
        at += n.max(1);
        o
    };
    let (t, ns, nl, nc) = (p.n_buckets, p.n_slots, p.n_local, MAX_COLORS);
    p.o_bcount = take(t);
    p.o_boff = take(t + 1);
    p.o_bcur = take(t);
    p.o_bent = take(4 * p.n_segs);
    p.o_ccount = take(ns);
    p.o_coff = take(ns + 1);
    p.o_ncount = take(nl);
    p.o_noff = take(nl + 1);
    p.o_ncur = take(nl);
    p.o_color = take(ns);
    p.o_lcount = take(nc + 1);
    p.o_loff = take(nc + 2);
    p.o_lcur = take(nc + 1);
    p.o_list = take(ns);
    p.o_iface = take(p.n_ifaces + 1);
    p.o_act = take(ns);
    p.o_mask = take(nl);
    p.o_aflag = take(ns);
    p.o_aoff = take(ns + 1);
    p.o_alist = take(ns);
    p.o_lprev = take(2 * ns);
    p.o_nlist = take(nl);
    p.o_dvp = take(2 * nl);
    // The one-workgroup solve's packed rows (none on the per-colour path).
    let one = p.multi == 0;
    p.o_cidx = if one { take(3 * ns) } else { 0 };
    let words = at;
    let mut f = 0u32;
    let mut ftake = |n: u32| {
        let o = f;
        f += n.max(1);
        o
    };
    p.f_box = ftake(p.n_segs);
    p.f_usearch = ftake(nl);
    p.f_rp = ftake(ns);
    p.f_wp = ftake(nl.div_ceil(CG));
    // Friction partials per slot run (force along the tangents, work, its part after t_n).
    p.f_rf = if p.friction != 0 { ftake(ns) } else { 0 };
    p.f_row = if one { ftake(2 * ns) } else { 0 };
    p.f_frow = if one && p.friction != 0 { ftake(ns) } else { 0 };
    p.f_node = if one { ftake(nl + 1) } else { 0 };
    Workspace { words, vec4s: f }
}

/// Contact buffers, bind groups and the host's view of the device counters.
#[derive(Debug)]
pub struct ContactState {
    /// Parameters as last uploaded.
    pub params: ContactParams,
    set: ContactSet,
    /// Global index of each contact node.
    nodes: Vec<u32>,
    /// Interface names (history columns).
    pub names: Vec<String>,
    /// Counters as last read back.
    pub counters: ContactCounters,
    pub(crate) ctl: wgpu::Buffer,
    grow_buf: wgpu::Buffer,
    pub(crate) history: wgpu::Buffer,
    ind: wgpu::Buffer,
    _index: wgpu::Buffer,
    /// (binding, buffer) of the bind group, to rebuild it when the candidate buffer grows.
    entries: Vec<(u32, wgpu::Buffer)>,
    bind: wgpu::BindGroup,
    ind_bind: wgpu::BindGroup,
    /// Grow events so far (candidate buffer, colours recorded, colouring rounds).
    pub grows: u32,
    /// The stage in one workgroup before the search and one after it ([`one`]).
    one: bool,
}

fn make_bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    entries: &[(u32, wgpu::Buffer)],
) -> wgpu::BindGroup {
    let list: Vec<wgpu::BindGroupEntry<'_>> = entries
        .iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: if *binding == 17 {
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(16),
                })
            } else {
                buffer.as_entire_binding()
            },
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("contact"),
        layout,
        entries: &list,
    })
}

/// Choices of the contact stage a caller may make (tests, benchmarks); the defaults decide by
/// adapter and size.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ContactOptions {
    /// The per-colour solve path (`Some(true)`) or one workgroup (`Some(false)`); `None`:
    /// [`multi_path`].
    pub multi: Option<bool>,
    /// On the one-workgroup path, the active-set re-checks as their own dispatches over many
    /// workgroups (`Some(true)`) or inside the solve's workgroup (`Some(false)`); `None`:
    /// [`split_path`]. The same constraints and arithmetic either way: the same bits on
    /// lavapipe. On an H100 the two kernels round apart, the sweeps then stop in other sweeps,
    /// and the striker test's displacements differ by 1.5e-7 m: about as far as either path
    /// lies from the f64 CPU reference.
    pub split: Option<bool>,
    /// The contact stage in one workgroup before the search and one after it (`Some(true)`;
    /// the one-workgroup solve with its re-checks inside), or the per-item kernels
    /// (`Some(false)`); `None`: [`one::one_path`] where neither `multi` nor `split` is asked
    /// for. The same bits either way.
    pub one: Option<bool>,
    /// Plain projected Gauss-Seidel sweeps on the one-workgroup path (`true`) instead of the
    /// extrapolated ones (the default, as on the CPU reference); for comparisons.
    pub plain_sweeps: bool,
    /// Initial candidate capacity (words); `None`: 4 per slot, at least 1024. A search that
    /// needs more grows the buffer.
    pub candidate_capacity: Option<u32>,
    /// Threads of the one-workgroup contact kernels (the search's scans, the one-workgroup
    /// solve, the reports' end), a power of two from 8 to 256; `None`: [`one_group`]. Every
    /// size gives the same node bits (their sums are of integers, or per constraint within a
    /// colour); only the reports' float sums change order.
    pub group: Option<u32>,
}

/// Threads of the one-workgroup contact kernels on an adapter of `device_type`: 256 on GPUs, 8
/// on CPU adapters. On lavapipe one workgroup runs on one core in lane groups of 8, and each
/// barrier of a larger group switches between them: the 10^5-element striker's solve took
/// 1.78 ms a step with 64 threads, 1.24 ms with 8 (BENCHMARKS.md, session 18).
pub fn one_group(device_type: wgpu::DeviceType) -> u32 {
    if device_type == wgpu::DeviceType::Cpu {
        8
    } else {
        256
    }
}

/// How a scene's contact stage is solved and dispatched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Path {
    /// The per-colour solve path (else one workgroup).
    pub multi: bool,
    /// On the one-workgroup path, the re-checks as their own dispatches.
    pub split: bool,
    /// On the one-workgroup path, extrapolated sweeps.
    pub extrapolate: bool,
    /// The stage in one workgroup before the search and one after it ([`one`]).
    pub one: bool,
}

impl Path {
    /// The path `options` ask for, the rest by [`multi_path`], [`split_path`] and
    /// [`one::one_path`] for `nodes` contact nodes and `slots` slots.
    ///
    /// # Errors
    /// [`Error::Gpu`] when `options` ask for one workgroup with the per-colour path or split
    /// re-checks.
    pub fn choose(
        options: &ContactOptions,
        nodes: usize,
        slots: usize,
        device_type: wgpu::DeviceType,
    ) -> Result<Path> {
        let multi = options
            .multi
            .unwrap_or_else(|| multi_path(slots, device_type));
        let split = options
            .split
            .unwrap_or_else(|| split_path(slots, device_type));
        let one = options
            .one
            .unwrap_or_else(|| !multi && !split && one::one_path(nodes, device_type));
        if one && (multi || split) {
            return Err(Error::Gpu(
                "the contact stage in one workgroup takes neither the per-colour solve nor split \
                 re-checks"
                    .into(),
            ));
        }
        Ok(Path {
            multi,
            split,
            extrapolate: !options.plain_sweeps,
            one,
        })
    }
}

/// Whether the per-colour path is used for `slots` slots on an adapter of `device_type`.
pub fn multi_path(slots: usize, device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu && slots >= solve::MULTI_SLOTS
}

/// Whether the one-workgroup solve leaves its re-checks to their own dispatches, for `slots`
/// slots on an adapter of `device_type` (see [`solve::SPLIT_SLOTS`]).
pub fn split_path(slots: usize, device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu && slots >= solve::SPLIT_SLOTS
}

impl ContactState {
    /// Buffers of `set` (the model's contacts); `alloc` records each buffer for the plan report.
    /// `path`: the solve path and how the stage is dispatched.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &wgpu::Device,
        kernels: &ContactKernels,
        model: &Model,
        set: ContactSet,
        shared: Shared<'_>,
        row_capacity: u32,
        path: Path,
        candidate_capacity: Option<u32>,
        alloc: &mut Alloc<'_>,
    ) -> Result<ContactState> {
        let Path {
            multi,
            split,
            extrapolate,
            one,
        } = path;
        let t = set.tables();
        let nl = t.nodes.len();
        let c_ref: Vec<[f32; 4]> = t
            .reference
            .iter()
            .zip(&t.inv_mass)
            .map(|(x, im)| [x[0] as f32, x[1] as f32, im[0] as f32, im[1] as f32])
            .collect();
        let node_words: Vec<[u32; 2]> = t
            .nodes
            .iter()
            .zip(&t.mass)
            .map(|(&g, &m)| [g, (m as f32).to_bits()])
            .collect();
        let slots: Vec<GpuSlot> = t
            .slots
            .iter()
            .map(|s| GpuSlot {
                info: s.interface
                    | (u32::from(s.penalty) << 16)
                    | (u32::from(s.wall) << 17)
                    | (u32::from(s.second_is_slave) << 18)
                    | (u32::from(s.group) << 19)
                    | (u32::from(s.self_contact) << 20)
                    | (u32::from(s.perturbed) << 21),
                s: s.node,
                np: s.neighbours[0],
                nn: s.neighbours[1],
                normal: s.normal.map(|x| x as f32),
                point: s.point.map(|x| x as f32),
                k: s.stiffness as f32,
                pass: s.pass,
                body: s.body,
                mu: s.friction as f32,
                kt: s.friction_stiffness as f32,
                ps: s.neighbour_slots[0],
                ns: s.neighbour_slots[1],
                ar: s.augmentation as f32,
            })
            .collect();
        let segs: Vec<GpuSegment> = t
            .segments
            .iter()
            .map(|s| GpuSegment {
                a: s.nodes[0],
                b: s.nodes[1],
                k: s.stiffness as f32,
                pass: s.pass,
                body: s.body,
                _pad: [0; 3],
            })
            .collect();
        let names = set.names();
        let ni = names.len() as u32;
        if ni > 0xffff {
            return Err(Error::Gpu(format!(
                "the GPU backend supports at most 65535 contacts and walls (scene has {ni})"
            )));
        }
        // Each interface's slots are contiguous (passes, then walls, in interface order).
        let mut iface = vec![u32::MAX; ni as usize + 1];
        for (k, s) in t.slots.iter().enumerate().rev() {
            iface[s.interface as usize] = k as u32;
        }
        iface[ni as usize] = slots.len() as u32;
        for f in (0..ni as usize).rev() {
            if iface[f] == u32::MAX {
                iface[f] = iface[f + 1];
            }
        }
        if t.slots.windows(2).any(|w| w[1].interface < w[0].interface) {
            return Err(Error::Gpu(
                "contact slots are not grouped by interface".into(),
            ));
        }
        // Words per history row: the contact energy, with friction the friction work, then per
        // interface fx, fy, the largest penetration, the active nodes and with friction ft.
        let friction = t.slots.iter().any(|s| s.friction > 0.0);
        let hist_stride = if friction { 2 + 5 * ni } else { 1 + 4 * ni };
        let n_slots = slots.len() as u32;
        let n_segs = segs.len() as u32;
        let cand_capacity = candidate_capacity.unwrap_or((4 * n_slots).max(1024)).max(1);
        let mut params = ContactParams {
            n_local: nl as u32,
            n_slots,
            n_segs,
            n_ifaces: ni,
            margin: t.margin as f32,
            max_sweeps: if multi {
                solve::MULTI_SWEEPS
            } else {
                solve::MAX_SWEEPS
            },
            multi: u32::from(multi),
            hist_stride,
            row_capacity,
            n_buckets: (2 * n_segs).max(64).next_power_of_two(),
            cand_capacity,
            adj_capacity: n_slots + 2 * cand_capacity,
            jp_rounds: FIRST_ROUNDS,
            colors_recorded: if multi { 8 } else { 0 },
            one: 1.0,
            n_nodes: model.node_count() as u32,
            tolerance: (solve::TOLERANCE * t.margin) as f32,
            friction: u32::from(friction),
            split: u32::from(split && !multi),
            extrapolate: u32::from(extrapolate && !multi),
            ..Default::default()
        };
        let work = layout_workspace(&mut params);
        let mut ws_init = vec![0u32; work.words as usize];
        ws_init[params.o_iface as usize..params.o_iface as usize + iface.len()]
            .copy_from_slice(&iface);
        // Per node: (u_n, trial u), (v_free, v^{n-1/2}), (v kept for the next step, dv).
        let init_pv: Vec<[f32; 4]> = t
            .nodes
            .iter()
            .flat_map(|&g| {
                let v = model.velocity[g as usize];
                [[0.0; 4], [0.0; 4], [v[0] as f32, v[1] as f32, 0.0, 0.0]]
            })
            .collect();
        use wgpu::BufferUsages as U;
        let st = U::STORAGE;
        let nodes_buf = alloc.init("contact_nodes", bytemuck::cast_slice(&node_words), st);
        let ref_buf = alloc.init("contact_reference", bytemuck::cast_slice(&c_ref), st);
        let slot_words = if slots.is_empty() {
            vec![GpuSlot::default()]
        } else {
            slots.clone()
        };
        let slots_buf = alloc.init("contact_slots", bytemuck::cast_slice(&slot_words), st);
        // Storage bindings may not be empty: a scene with walls only binds one unused segment.
        let seg_words = if segs.is_empty() {
            vec![GpuSegment::default()]
        } else {
            segs.clone()
        };
        let segs_buf = alloc.init("contact_segments", bytemuck::cast_slice(&seg_words), st);
        let pv = alloc.init("contact_nodal", bytemuck::cast_slice(&init_pv), st);
        let cons = alloc.init(
            "contact_constraints",
            &vec![0u8; (CONS_SIZE as usize) * slots.len().max(1)],
            st,
        );
        let mut ctl_init = vec![0u8; CTL_SIZE as usize];
        ctl_init[..PARAMS_SIZE as usize].copy_from_slice(bytemuck::bytes_of(&params));
        let ctl = alloc.init("contact_state", &ctl_init, st | U::COPY_SRC | U::COPY_DST);
        let ws = alloc.init(
            "contact_workspace",
            bytemuck::cast_slice(&ws_init),
            st | U::COPY_SRC,
        );
        let grow_buf = alloc.init(
            "contact_candidates",
            &vec![0u8; 4 * (params.cand_capacity + params.adj_capacity) as usize],
            st | U::COPY_SRC,
        );
        let fws = alloc.init(
            "contact_workspace_f32",
            &vec![0u8; 16 * work.vec4s as usize],
            st,
        );
        let history = alloc.init(
            "contact_history",
            &vec![0u8; 4 * (row_capacity * hist_stride + 4 * (ni + 2)) as usize],
            st | U::COPY_SRC,
        );
        let ind = alloc.init(
            "contact_indirect",
            &vec![0u8; 12 * (ACTIVE_ENTRY as usize + 1)],
            st | U::INDIRECT,
        );
        let entries_n = ROUND_ENTRIES
            + if multi {
                MAX_SWEEP_SLOTS as u64 * MAX_COLORS as u64
            } else {
                0
            };
        let mut index_bytes = vec![0u8; (entries_n * INDEX_STRIDE) as usize];
        for e in 0..entries_n {
            let v: [u32; 4] = if e < ROUND_ENTRIES {
                [e as u32, 0, 0, 0]
            } else {
                let r = (e - ROUND_ENTRIES) as u32;
                [r % MAX_COLORS, r / MAX_COLORS, 0, 0]
            };
            let at = (e * INDEX_STRIDE) as usize;
            index_bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&v));
        }
        let index = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("contact_index"),
            contents: &index_bytes,
            usage: U::UNIFORM,
        });
        alloc.record("contact_index", index.size());
        let entries = vec![
            (1, shared.ctrl.clone()),
            (2, shared.nodes.clone()),
            (3, shared.v_prev.clone()),
            (4, shared.sample_src.clone()),
            (5, nodes_buf),
            (6, ref_buf),
            (7, slots_buf),
            (8, segs_buf),
            (9, pv),
            (11, cons),
            (12, ctl.clone()),
            (13, ws),
            (14, grow_buf.clone()),
            (15, fws),
            (16, history.clone()),
            (17, index.clone()),
        ];
        let bind = make_bind(device, &kernels.layout, &entries);
        let ind_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("contact_indirect"),
            layout: &kernels.ind_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: ind.as_entire_binding(),
            }],
        });
        Ok(ContactState {
            params,
            set,
            nodes: t.nodes,
            names,
            counters: ContactCounters::default(),
            ctl,
            grow_buf,
            history,
            ind,
            _index: index,
            entries,
            bind,
            ind_bind,
            grows: 0,
            one,
        })
    }

    /// The penalty springs' stable step and what sets it.
    pub fn penalty_step(&self) -> Option<(f64, &str)> {
        self.set.penalty_step()
    }

    /// Global node indices of the contact nodes.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes
    }

    /// The buffer at `binding` of the contact bind group (test hooks).
    pub(crate) fn binding(&self, binding: u32) -> Option<&wgpu::Buffer> {
        self.entries.iter().find(|e| e.0 == binding).map(|e| &e.1)
    }

    /// Whether the per-colour solve path is in use.
    pub fn multi(&self) -> bool {
        self.params.multi != 0
    }

    /// Whether the stage runs in one workgroup before the search and one after it ([`one`]).
    pub fn one(&self) -> bool {
        self.one
    }

    /// Broad-phase searches so far (as last read back).
    pub fn searches(&self) -> u64 {
        self.counters.searches as u64
    }

    /// Records the contact stage of a step.
    pub fn record(&self, k: &ContactKernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_parts(k, pass, PART_ALL);
    }

    /// Records the parts of the contact stage named by `parts` (a mask of [`PART_PREP`],
    /// [`PART_SEARCH`], [`PART_NARROW`], [`PART_SOLVE`], [`PART_REPORT`]), in stage order: the
    /// whole stage with [`PART_ALL`]; one part alone only for timing its kernels (the bench's
    /// contact shares), since alone it works on whatever the other parts left. In one
    /// workgroup ([`ContactState::one`]) the narrow part is the whole stage after the search,
    /// and the solve and report parts record nothing.
    pub fn record_parts(&self, k: &ContactKernels, pass: &mut wgpu::ComputePass<'_>, parts: u32) {
        let p = &self.params;
        let g = |n: u32| n.div_ceil(CG).max(1);
        // Group 0 is set once (offset 0) and again only where its index offset changes: every
        // contact pipeline shares its layout, so it stays bound across pipelines.
        let bind = |pass: &mut wgpu::ComputePass<'_>, entry: u64| {
            pass.set_bind_group(0, &self.bind, &[(entry * INDEX_STRIDE) as u32]);
        };
        let direct = |pass: &mut wgpu::ComputePass<'_>, pl: &wgpu::ComputePipeline, n: u32| {
            pass.set_pipeline(pl);
            pass.dispatch_workgroups(n, 1, 1);
        };
        bind(pass, 0);
        pass.set_bind_group(1, &self.ind_bind, &[]);
        if parts & PART_PREP != 0 {
            if self.one {
                direct(pass, &k.prep_one, 1);
            } else {
                direct(pass, &k.prep, g(p.n_local));
                direct(pass, &k.plan, 1);
            }
        }
        for (e, pl) in k.search.iter().enumerate() {
            if parts & PART_SEARCH == 0 {
                break;
            }
            // The one-workgroup solve colours the step's constraints itself: no colouring of
            // the slots at the search.
            if p.multi == 0 && e >= 11 {
                break;
            }
            if e == 11 {
                pass.set_pipeline(pl);
                for r in 0..p.jp_rounds {
                    bind(pass, r as u64);
                    pass.dispatch_workgroups_indirect(&self.ind, 12 * e as u64);
                }
                bind(pass, 0);
                continue;
            }
            if e == 13 {
                direct(pass, &k.scan_lists, 1);
            }
            pass.set_pipeline(pl);
            pass.dispatch_workgroups_indirect(&self.ind, 12 * e as u64);
        }
        if self.one {
            // Narrow phase to reports in one dispatch (timed as the narrow part).
            if parts & PART_NARROW != 0 {
                direct(pass, &k.contact_one, 1);
            }
            return;
        }
        let active = |pass: &mut wgpu::ComputePass<'_>, pl: &wgpu::ComputePipeline| {
            pass.set_pipeline(pl);
            pass.dispatch_workgroups_indirect(&self.ind, 12 * ACTIVE_ENTRY as u64);
        };
        if parts & PART_NARROW != 0 {
            active(pass, &k.narrow);
            direct(pass, &k.gather, g(p.n_local));
        }
        let solve = parts & PART_SOLVE != 0;
        if solve && p.multi == 0 && p.split != 0 {
            // Round r of the solve, then its re-check r over the active slots (index entry r).
            let rounds = crate::contact::ACTIVE_SET_ROUNDS as u64;
            for r in 0..=rounds {
                bind(pass, r);
                direct(pass, &k.solve_one, 1);
                if r < rounds {
                    active(pass, &k.recheck_active);
                }
            }
            bind(pass, 0);
        } else if solve && p.multi == 0 {
            direct(pass, &k.solve_one, 1);
        } else if solve {
            let rounds = MAX_SWEEP_SLOTS / p.max_sweeps;
            for r in 0..rounds {
                pass.set_pipeline(&k.sweep_color);
                for s in 0..p.max_sweeps {
                    let q = r * p.max_sweeps + s;
                    for c in 0..p.colors_recorded {
                        bind(pass, ROUND_ENTRIES + (q * MAX_COLORS + c) as u64);
                        pass.dispatch_workgroups_indirect(&self.ind, 12 * (14 + c as u64));
                    }
                }
                if r + 1 < rounds {
                    pass.set_pipeline(&k.recheck);
                    bind(pass, r as u64);
                    pass.dispatch_workgroups(g(p.n_slots), 1, 1);
                }
            }
            bind(pass, 0);
        }
        if parts & PART_REPORT != 0 {
            direct(pass, &k.finish, g(p.n_local));
            active(pass, &k.report_slots);
            direct(pass, &k.report_end, 1);
        }
    }

    /// Gives the candidate buffer room for `cap` candidates (a new, zeroed buffer, bound in
    /// place of the old one).
    pub(crate) fn resize_candidates(
        &mut self,
        device: &wgpu::Device,
        kernels: &ContactKernels,
        cap: u32,
    ) {
        self.params.cand_capacity = cap;
        self.params.adj_capacity = self.params.n_slots + 2 * cap;
        let bytes = 4 * (cap as u64 + self.params.adj_capacity as u64);
        self.grow_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("contact_candidates"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        for e in &mut self.entries {
            if e.0 == 14 {
                e.1 = self.grow_buf.clone();
            }
        }
        self.bind = make_bind(device, &kernels.layout, &self.entries);
    }

    /// The candidate buffer now in use.
    pub(crate) fn candidates_buffer(&self) -> &wgpu::Buffer {
        &self.grow_buf
    }

    /// After a step stopped with [`STATE_SEARCH_GROW`] (`counters` just read back): enlarges what
    /// the search asked for, and marks a search due so that the resumed step searches again.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the colouring needs more than [`MAX_COLORS`] colours.
    pub(crate) fn grow(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &ContactKernels,
    ) -> Result<()> {
        let c = self.counters;
        if c.grow & GROW_CANDIDATES != 0 {
            let need = c.need_cand.max(self.params.cand_capacity + 1);
            let cap = (need + need / 2).next_power_of_two();
            self.resize_candidates(device, kernels, cap);
        }
        if c.grow & GROW_ROUNDS != 0 {
            if self.params.jp_rounds >= MAX_COLORS {
                return Err(Error::Gpu(format!(
                    "contact colouring needs more than {MAX_COLORS} colours: the candidate \
                     pairs are too dense (a node near very many segments)"
                )));
            }
            self.params.jp_rounds = (2 * self.params.jp_rounds).min(MAX_COLORS);
        }
        if c.grow & GROW_COLORS != 0 {
            self.params.colors_recorded = c.n_colors.min(MAX_COLORS);
        }
        self.grows += 1;
        queue.write_buffer(&self.ctl, 0, bytemuck::bytes_of(&self.params));
        // Counters: due = 1 (offset 0), grow = 0 (offset 32).
        queue.write_buffer(&self.ctl, PARAMS_SIZE, bytemuck::bytes_of(&1u32));
        queue.write_buffer(&self.ctl, PARAMS_SIZE + 32, bytemuck::bytes_of(&0u32));
        Ok(())
    }
}
